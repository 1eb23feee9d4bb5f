//! Per-pixel sample generators: stratified jitter (the seed report's sampler) and Owen-scrambled
//! Sobol (Burley 2020: `sobol::sobol_pair`).
//!
//! A `Sampler` is created for one (pixel, sample index) and hands out the sample's dimensions in a
//! fixed order: the pixel position, the lens position, then anything the integrator asks for.
//! Its state depends only on (seed, pixel, index), so images do not depend on thread count or on
//! how samples are split into passes.

use super::sobol::{sobol_first, sobol_pair};
use super::{Rng32, SeedPrefix, hash_seed, part_mix, permutation_element};
use glam::Vec2;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SamplerKind {
    /// N x N jittered strata for the pixel and (in a shuffled order) for the lens.
    #[default]
    Jittered,
    /// Owen-scrambled Sobol points, each 2-D pair independently shuffled.
    Sobol,
}

impl std::str::FromStr for SamplerKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "jittered" => Ok(SamplerKind::Jittered),
            "sobol" => Ok(SamplerKind::Sobol),
            _ => Err(format!("unknown sampler `{s}` (expected `jittered` or `sobol`)")),
        }
    }
}

pub struct Sampler {
    kind: SamplerKind,
    rng: Rng32,
    /// `hash_seed` after the pixel's seed: the sample's streams hash on from it.
    pixel: SeedPrefix,
    index: u32,
    /// Strata per axis for the jittered sampler.
    strata: u32,
    /// Which 2-D pair is next (0 = pixel, 1 = lens, ...).
    pair: u32,
    /// The scramble of the pixel pair (`scramble_mixed` of pair 0), which a `PixelSampler` keeps from one
    /// sample of the pixel to the next.
    pixel_scramble: u32,
    /// `part_mix` of the sample's group (`group_of`), for `scramble_mixed`.
    group_mix: u64,
}

/// Sobol dimensions available per seed; sample indices beyond 2^16 move on to a fresh seed.
const SOBOL_INDEX_BITS: u32 = 16;

/// The samplers of one pixel's samples, made one after another: what they share (the pixel's
/// hash prefix, the pixel pair's stratum permutation or Sobol scramble for a run of indices) is
/// computed once rather than per sample. Each `sampler(index)` equals `Sampler::new` with the
/// same arguments.
pub struct PixelSampler {
    kind: SamplerKind,
    pixel: SeedPrefix,
    strata: u32,
    /// The set (jittered) or block (Sobol) whose pixel-pair scramble is `scramble`.
    group: Option<u32>,
    scramble: u32,
    /// `part_mix` of the group (`scramble_mixed`).
    group_mix: u64,
}

impl PixelSampler {
    #[inline]
    pub fn new(kind: SamplerKind, pixel_seed: u64, strata: u32) -> Self {
        let pixel = SeedPrefix::new(&[pixel_seed]);
        PixelSampler { kind, pixel, strata: strata.max(1), group: None, scramble: 0, group_mix: 0 }
    }

    /// The sampler of sample `index` of this pixel.
    #[inline(always)]
    pub fn sampler(&mut self, index: u32) -> Sampler {
        let group = group_of(self.kind, index, self.strata);
        if self.group != Some(group) {
            self.group = Some(group);
            self.group_mix = part_mix(group as u64);
            self.scramble = scramble_mixed(self.pixel, 0, self.group_mix);
        }
        Sampler::with_scramble(self.kind, self.pixel, index, self.strata, self.scramble, self.group_mix)
    }
}

/// Which run of sample indices shares one stratum permutation (jittered: the set of N^2) or one
/// Sobol scramble (the block of 2^16).
#[inline]
fn group_of(kind: SamplerKind, index: u32, strata: u32) -> u32 {
    match kind {
        SamplerKind::Jittered => {
            let n2 = strata * strata;
            // Strata counts are mostly powers of two, whose divisions are shifts.
            if strata.is_power_of_two() { index >> n2.trailing_zeros() } else { index / n2 }
        }
        SamplerKind::Sobol => index >> SOBOL_INDEX_BITS,
    }
}

/// The seed of pair `pair`'s stratum permutation (jittered) or Sobol scramble in its group:
/// `hash(pixel, pair, group)` (the tests' `scramble`), with the group's part mixed already
/// (`part_mix(group)`, kept by the sampler) and the pair's read from `PAIR_MIX` when it is
/// there: two of the hash's four mixing rounds, each a chain of dependent multiplies, leave the
/// path of every pair.
#[inline(always)]
fn scramble_mixed(pixel: SeedPrefix, pair: u32, group_mix: u64) -> u32 {
    let pair_mix = PAIR_MIX.get(pair as usize).copied().unwrap_or_else(|| part_mix(pair as u64));
    (pixel.then_mixed(pair_mix).then_mixed(group_mix).0 >> 32) as u32
}

/// `part_mix` of the pair numbers a path uses (beyond them it is computed).
static PAIR_MIX: [u64; 64] = {
    let mut t = [0u64; 64];
    let mut p = 0;
    while p < 64 {
        t[p] = part_mix(p as u64);
        p += 1;
    }
    t
};

impl Sampler {
    /// The sampler for sample `index` of pixel (x, y). `strata` is N for N x N jittered strata;
    /// indices k N^2 .. (k+1) N^2 - 1 form the k-th stratified set.
    pub fn new(kind: SamplerKind, seed: u64, x: u32, y: u32, index: u32, strata: u32) -> Self {
        PixelSampler::new(kind, Self::pixel_seed(seed, x, y), strata).sampler(index)
    }

    /// The seed of pixel (x, y)'s samples: computed once per pixel by callers that take many
    /// samples of it (`PixelSampler`).
    #[inline]
    pub fn pixel_seed(seed: u64, x: u32, y: u32) -> u64 {
        hash_seed(&[seed, x as u64, y as u64])
    }

    #[inline]
    fn with_scramble(
        kind: SamplerKind,
        pixel: SeedPrefix,
        index: u32,
        strata: u32,
        pixel_scramble: u32,
        group_mix: u64,
    ) -> Self {
        let rng = Rng32::new(pixel.hash(&[index as u64]));
        Sampler { kind, rng, pixel, index, strata, pair: 0, pixel_scramble, group_mix }
    }

    /// Position within the pixel, in [0,1)^2.
    pub fn pixel(&mut self) -> Vec2 {
        debug_assert_eq!(self.pair, 0, "pixel() must be the first request");
        self.next_pair(true)
    }

    /// Position on the lens, in [0,1)^2, stratified like the pixel samples but decorrelated from
    /// them (a different permutation of the strata, or an independently shuffled Sobol pair).
    pub fn lens(&mut self) -> Vec2 {
        self.next_pair(true)
    }

    /// Moves past the lens sample without making it (for a camera that reads none), leaving
    /// the sampler exactly where `lens` would: the jittered sampler's stratum permutation is
    /// most of a pinhole camera sample's cost.
    #[inline]
    pub fn skip_lens(&mut self) {
        self.pair += 1;
        if self.kind == SamplerKind::Jittered {
            self.rng.uniform2();
        }
    }

    /// A further 2-D sample for the integrator (uniform, not stratified, with the jittered
    /// sampler: two numbers of the pixel sample's stream, drawn inline).
    #[inline]
    pub fn next_2d(&mut self) -> Vec2 {
        if self.kind == SamplerKind::Jittered {
            self.pair += 1;
            return self.rng.uniform2();
        }
        self.next_pair(false)
    }

    /// A further 1-D sample: the first coordinate of `next_2d` (a Sobol pair's second is not
    /// worked out).
    #[inline]
    pub fn next_1d(&mut self) -> f32 {
        if self.kind == SamplerKind::Jittered {
            return self.next_2d().x;
        }
        self.next_sobol_first()
    }

    /// `next_pair(false).x` of a Sobol sampler. Out of line, as `next_pair` is.
    #[inline(never)]
    fn next_sobol_first(&mut self) -> f32 {
        let scramble = self.next_scramble();
        sobol_first(self.sobol_index(), scramble).min(ONE_MINUS_EPS)
    }

    /// The plain random stream of this pixel sample, for decisions that need no stratification.
    pub fn rng(&mut self) -> &mut Rng32 {
        &mut self.rng
    }

    /// A stream of this pixel sample's own beside the sampler's, for draws whose count varies
    /// from sample to sample (a heterogeneous medium's tracking steps): seeded by (pixel seed,
    /// sample index, `tag`), so drawing from it moves none of the sampler's dimensions and the
    /// numbers depend on nothing but the sample.
    #[inline]
    pub fn side_stream(&self, tag: u64) -> Rng32 {
        Rng32::new(self.pixel.hash(&[self.index as u64, tag]))
    }

    /// The next pair's scramble (a stratum permutation's, or a Sobol sequence's seed).
    #[inline(always)]
    fn next_scramble(&mut self) -> u32 {
        let pair = self.pair;
        self.pair += 1;
        if pair == 0 { self.pixel_scramble } else { scramble_mixed(self.pixel, pair, self.group_mix) }
    }

    /// The sample's index in its Sobol sequences.
    #[inline(always)]
    fn sobol_index(&self) -> u32 {
        self.index & ((1 << SOBOL_INDEX_BITS) - 1)
    }

    #[inline(never)]
    fn next_pair(&mut self, stratified_pair: bool) -> Vec2 {
        if self.kind == SamplerKind::Jittered && !stratified_pair {
            self.pair += 1;
            return self.rng.uniform2();
        }
        let scramble = self.next_scramble();
        match self.kind {
            SamplerKind::Jittered => {
                // Samples come in sets of N^2, one per stratum. Within a set, each pair visits
                // the strata in its own per-pixel random order, so a partial set (a time budget,
                // an interrupted render, spp below N^2) is spread over the pixel rather than
                // bunched in its first rows, and pixel and lens strata are not matched one to
                // one (Suffern ch. 5 shuffles the same way).
                let n2 = self.strata * self.strata;
                // Strata counts are mostly powers of two, whose divisions are shifts (a divide
                // is a tenth of a pinhole camera sample).
                let pow2 = self.strata.is_power_of_two();
                let k = if pow2 { self.index & (n2 - 1) } else { self.index % n2 };
                let s = permutation_element(k, n2, scramble);
                let (sx, sy) = if pow2 {
                    (s & (self.strata - 1), s >> self.strata.trailing_zeros())
                } else {
                    (s % self.strata, s / self.strata)
                };
                let j = self.rng.uniform2();
                let inv = 1.0 / self.strata as f32;
                Vec2::new(((sx as f32 + j.x) * inv).min(ONE_MINUS_EPS), ((sy as f32 + j.y) * inv).min(ONE_MINUS_EPS))
            }
            SamplerKind::Sobol => {
                let (x, y) = sobol_pair(self.sobol_index(), scramble);
                Vec2::new(x.min(ONE_MINUS_EPS), y.min(ONE_MINUS_EPS))
            }
        }
    }
}

const ONE_MINUS_EPS: f32 = 1.0 - f32::EPSILON / 2.0;

#[cfg(test)]
mod tests {
    use super::*;

    /// The definition `scramble_mixed` computes faster: the pixel's seed list followed by the
    /// pair and the group, hashed.
    fn scramble(pixel: SeedPrefix, pair: u32, group: u32) -> u32 {
        (pixel.hash(&[pair as u64, group as u64]) >> 32) as u32
    }

    /// The scramble with premixed parts is the scramble, inside the table of pair parts and
    /// beyond it.
    #[test]
    fn premixed_scrambles_are_the_scrambles() {
        let pixel = SeedPrefix::new(&[Sampler::pixel_seed(9, 3, 4)]);
        for group in [0u32, 1, 7, 1 << 20] {
            for pair in (0..200).chain([u32::MAX]) {
                let mixed = scramble_mixed(pixel, pair, part_mix(group as u64));
                assert_eq!(mixed, scramble(pixel, pair, group), "pair {pair} group {group}");
            }
        }
    }

    /// Skipping the lens sample leaves every later sample as drawing it does.
    #[test]
    fn skip_lens_keeps_the_stream() {
        for kind in [SamplerKind::Jittered, SamplerKind::Sobol] {
            for index in [0, 5, 17, 100] {
                let mut a = Sampler::new(kind, 3, 4, 5, index, 4);
                let mut b = Sampler::new(kind, 3, 4, 5, index, 4);
                assert_eq!(a.pixel(), b.pixel());
                a.lens();
                b.skip_lens();
                for _ in 0..3 {
                    assert_eq!(a.next_2d(), b.next_2d());
                    assert_eq!(a.rng().next_u32(), b.rng().next_u32());
                }
            }
        }
    }

    /// One pixel's samplers made in turn, across sets and Sobol blocks, are those made alone.
    #[test]
    fn a_pixel_sampler_makes_the_samplers_new_makes() {
        for kind in [SamplerKind::Jittered, SamplerKind::Sobol] {
            for strata in [1, 3, 4] {
                let mut pixel = PixelSampler::new(kind, Sampler::pixel_seed(9, 2, 7), strata);
                for index in (0..40).chain([65_530, 65_536, 65_537, 200_000, 7]) {
                    let mut a = pixel.sampler(index);
                    let mut b = Sampler::new(kind, 9, 2, 7, index, strata);
                    assert_eq!(a.pixel(), b.pixel());
                    assert_eq!(a.lens(), b.lens());
                    assert_eq!(a.next_2d(), b.next_2d());
                    assert_eq!(a.side_stream(3).next_u32(), b.side_stream(3).next_u32());
                }
            }
        }
    }

    fn check_stratified(kind: SamplerKind, n: u32, lens: bool) {
        for (x, y) in [(0, 0), (17, 3), (500, 900)] {
            let mut seen = vec![false; (n * n) as usize];
            let set = if kind == SamplerKind::Jittered { 2 } else { 0 };
            for i in set * n * n..(set + 1) * n * n {
                let mut s = Sampler::new(kind, 42, x, y, i, n);
                let mut p = s.pixel();
                if lens {
                    p = s.lens();
                }
                assert!(p.x >= 0.0 && p.x < 1.0 && p.y >= 0.0 && p.y < 1.0);
                let cell = (p.y * n as f32) as u32 * n + (p.x * n as f32) as u32;
                assert!(!seen[cell as usize], "{kind:?} n={n} lens={lens}: two samples in cell {cell}");
                seen[cell as usize] = true;
            }
        }
    }

    #[test]
    fn jittered_pixel_and_lens_samples_are_stratified() {
        for n in [1, 2, 3, 5, 8] {
            check_stratified(SamplerKind::Jittered, n, false);
            check_stratified(SamplerKind::Jittered, n, true);
        }
    }

    #[test]
    fn sobol_first_n2_points_are_stratified() {
        for n in [2, 4, 8, 16] {
            check_stratified(SamplerKind::Sobol, n, false);
            check_stratified(SamplerKind::Sobol, n, true);
        }
    }

    #[test]
    fn a_partial_jittered_set_is_spread_over_the_pixel() {
        // With 8 x 8 strata, the first 4 samples must not sit in the first row of strata: over
        // many pixels their mean is the pixel centre (standard error ~0.29/sqrt(4000) = 0.005).
        let mut sum = Vec2::ZERO;
        let n = 1000;
        for x in 0..n {
            for i in 0..4 {
                sum += Sampler::new(SamplerKind::Jittered, 5, x, 7, i, 8).pixel();
            }
        }
        let mean = sum / (4 * n) as f32;
        assert!((mean - Vec2::splat(0.5)).abs().max_element() < 0.025, "{mean}");
    }

    #[test]
    fn lens_is_decorrelated_from_pixel() {
        // Over many pixels the lens stratum must not equal the pixel stratum for every sample.
        let n = 4;
        let mut same = 0;
        let mut total = 0;
        for x in 0..50 {
            for i in 0..n * n {
                let mut s = Sampler::new(SamplerKind::Jittered, 1, x, 0, i, n);
                let p = s.pixel();
                let l = s.lens();
                let cell = |q: Vec2| (q.y * n as f32) as u32 * n + (q.x * n as f32) as u32;
                same += (cell(p) == cell(l)) as u32;
                total += 1;
            }
        }
        assert!(same < total / 4, "{same} of {total} lens samples share the pixel stratum");
    }

    #[test]
    fn samplers_are_deterministic() {
        let a: Vec<Vec2> = (0..8).map(|i| Sampler::new(SamplerKind::Sobol, 3, 4, 5, i, 2).next_2d()).collect();
        let b: Vec<Vec2> = (0..8).map(|i| Sampler::new(SamplerKind::Sobol, 3, 4, 5, i, 2).next_2d()).collect();
        assert_eq!(a, b);
    }
}
