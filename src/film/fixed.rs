//! Exact pixel sums. Each sample value is rounded once, towards zero, to a fixed-point number
//! with 48 fractional bits, and a pixel's sum is an integer. Integer addition is associative, so
//! a pixel's sum is the same bit for bit however its samples are split: into passes, over
//! threads, across a checkpoint and a resumed run, or over the machines of a render farm whose
//! partial sums `caustic merge` adds.
//!
//! Range: a sample's magnitude is capped at 2^46 (about 7e13, far above any radiance a scene
//! gives), so even 2^32 samples at the cap fit in an `i128`. Resolution: 2^-48 (3.6e-15) per
//! sample, below anything an f32 image can show next to a visible value.

use crate::math::Color;

/// The exact sum of a pixel's samples, per RGB channel, in units of 2^-48.
pub type FixedRgb = [i128; 3];

pub const FRACTION_BITS: u32 = 48;
const SCALE: f64 = (1u64 << FRACTION_BITS) as f64;
/// Largest sample magnitude kept exactly; larger values are clamped to it.
pub const MAX_SAMPLE: f32 = (1u64 << 46) as f32;

/// `v` in fixed point (NaN, which callers reject first, becomes 0).
#[inline]
pub fn to_fixed(v: f32) -> i128 {
    let x = v.clamp(-MAX_SAMPLE, MAX_SAMPLE) as f64 * SCALE;
    // f32 * 2^48 is exact in f64. Below 2^63 (values under 32768, nearly all samples) the
    // conversion through i64 is a single instruction and gives the same integer.
    if x.abs() < 9.0e18 { x as i64 as i128 } else { x as i128 }
}

#[inline]
pub fn to_fixed_rgb(c: Color) -> FixedRgb {
    [to_fixed(c.r()), to_fixed(c.g()), to_fixed(c.b())]
}

#[inline]
pub fn add_rgb(acc: &mut FixedRgb, v: &FixedRgb) {
    for (a, b) in acc.iter_mut().zip(v) {
        *a += *b;
    }
}

/// The mean of `n` samples whose exact sum is `sum` (black for none).
#[inline]
pub fn mean(sum: &FixedRgb, n: u32) -> Color {
    if n == 0 {
        return Color::ZERO;
    }
    // SCALE * n is exact in f64, so the only roundings are of the sum and of the quotient.
    let d = SCALE * n as f64;
    Color::new((sum[0] as f64 / d) as f32, (sum[1] as f64 / d) as f32, (sum[2] as f64 / d) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn exact_for_values_on_the_grid_and_clamped_beyond_the_cap() {
        assert_eq!(to_fixed(1.0), 1i128 << 48);
        assert_eq!(to_fixed(-0.5), -(1i128 << 47));
        assert_eq!(to_fixed(0.0), 0);
        assert_eq!(to_fixed(f32::NAN), 0);
        assert_eq!(to_fixed(1e30), to_fixed(MAX_SAMPLE));
        assert_eq!(to_fixed(MAX_SAMPLE), 1i128 << 94);
        // The slow path agrees with the fast one where both apply.
        let v = 30000.123f32;
        assert_eq!(to_fixed(v), (v as f64 * SCALE) as i128);
        assert_eq!(to_fixed(40000.5), (40000.5f64 * SCALE) as i128);
        // 2^32 samples at the cap cannot overflow.
        assert!((to_fixed(MAX_SAMPLE)).checked_mul(u32::MAX as i128).is_some());
    }

    proptest! {
        #[test]
        fn any_split_of_the_samples_gives_the_same_mean(
            values in prop::collection::vec(0.0f32..1e4, 1..40),
            cut in 0usize..40,
        ) {
            let cut = cut.min(values.len());
            let sum = |vs: &[f32]| vs.iter().map(|&v| to_fixed(v)).sum::<i128>();
            let whole = sum(&values);
            let (a, b) = values.split_at(cut);
            let mut rev = values.clone();
            rev.reverse();
            prop_assert_eq!(sum(a) + sum(b), whole);
            prop_assert_eq!(sum(&rev), whole);
            // The mean is within the fixed-point resolution of the exact one.
            let exact = values.iter().map(|&v| v as f64).sum::<f64>() / values.len() as f64;
            let m = mean(&[whole, 0, 0], values.len() as u32).r() as f64;
            prop_assert!((m - exact).abs() <= exact * 1e-6 + 1e-12);
        }
    }
}
