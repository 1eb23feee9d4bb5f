use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg32;

use super::*;

/// Largest relative deviation of a colour's chromaticity (each channel over the sum) from
/// that of white, (1/3, 1/3, 1/3).
fn chromaticity_error(c: Color) -> f64 {
    let [r, g, b] = c.to_array().map(f64::from);
    let sum = r + g + b;
    [r, g, b].iter().map(|v| (v / sum * 3.0 - 1.0).abs()).fold(0.0, f64::max)
}

/// Mean and standard deviation per channel of one path's estimate of `spectrum`'s colour over
/// `n` random wavelength samples.
fn estimate(
    n: usize,
    distribution: WavelengthDistribution,
    spectrum: impl Fn(&SampledWavelengths) -> SpectrumSample,
    terminate: bool,
) -> ([f64; 3], [f64; 3]) {
    let mut rng = Pcg32::seed_from_u64(7);
    let (mut sum, mut sum2) = ([0.0f64; 3], [0.0f64; 3]);
    for _ in 0..n {
        let mut wl = SampledWavelengths::sample_from(rng.random::<f32>(), distribution);
        if terminate {
            wl.terminate_secondary();
        }
        let c = spectrum(&wl).to_srgb(&wl).to_array();
        for k in 0..3 {
            sum[k] += c[k] as f64;
            sum2[k] += (c[k] as f64).powi(2);
        }
    }
    let mean = sum.map(|s| s / n as f64);
    let sd = std::array::from_fn(|k| (sum2[k] / n as f64 - mean[k] * mean[k]).max(0.0).sqrt());
    (mean, sd)
}

fn d65_light(wl: &SampledWavelengths) -> SpectrumSample {
    wl.map(d65)
}

#[test]
fn arithmetic_is_per_wavelength() {
    let a = SpectrumSample::new(1.0, 2.0, 3.0, 4.0);
    let b = SpectrumSample::splat(2.0);
    assert_eq!((a + b).to_array(), [3.0, 4.0, 5.0, 6.0]);
    assert_eq!((a - b).to_array(), [-1.0, 0.0, 1.0, 2.0]);
    assert_eq!((a * b).to_array(), [2.0, 4.0, 6.0, 8.0]);
    assert_eq!((a / 2.0).to_array(), [0.5, 1.0, 1.5, 2.0]);
    assert_eq!((2.0 * a)[3], 8.0);
    let mut c = a;
    c *= a;
    c += 1.0;
    assert_eq!(c.to_array(), [2.0, 5.0, 10.0, 17.0]);
    assert_eq!(a.average(), 2.5);
    assert_eq!((a.max_element(), a.min_element()), (4.0, 1.0));
    assert_eq!(a.safe_div(SpectrumSample::new(2.0, 0.0, 1.0, 0.0)).to_array(), [0.5, 0.0, 3.0, 0.0]);
    assert!(SpectrumSample::ZERO.is_black() && !a.is_black());
    assert_eq!(std::mem::size_of::<SpectrumSample>(), 16);
}

/// The hard-coded tanh values are those of the distribution's ends, its pdf integrates to 1,
/// and sampling is its inverse CDF: CDF(lambda(u)) = u, and the pdf is the CDF's slope.
#[test]
fn visible_distribution_is_normalised_and_inverted() {
    let (a, mu) = (VISIBLE_A as f64, VISIBLE_MU as f64);
    assert!(((a * (360.0 - mu)).tanh() - TANH_LO as f64).abs() < 1e-7);
    assert!(((a * (830.0 - mu)).tanh() - TANH_HI as f64).abs() < 1e-7);
    let integral: f64 = (0..47_000).map(|i| visible_pdf(360.0 + (i as f32 + 0.5) * 0.01) as f64 * 0.01).sum();
    assert!((integral - 1.0).abs() < 1e-4, "{integral}");
    let cdf = |l: f64| ((a * (l - mu)).tanh() - TANH_LO as f64) / (TANH_HI - TANH_LO) as f64;
    for i in 0..=100 {
        let u = (i as f32 / 100.0).min(0.999_999);
        let wl = SampledWavelengths::sample_from(u, WavelengthDistribution::Visible);
        let l = wl.lambda(0) as f64;
        assert!((cdf(l) - u as f64).abs() < 2e-5, "u {u}: cdf {}", cdf(l));
        let slope = (cdf(l + 0.01) - cdf(l - 0.01)) / 0.02;
        assert!((slope / wl.pdf()[0] as f64 - 1.0).abs() < 1e-3 || !(360.02..829.98).contains(&l));
    }
}

#[test]
fn secondary_wavelengths_are_the_hero_rotated() {
    let wl = SampledWavelengths::sample_from(0.1, WavelengthDistribution::Uniform);
    let step = (LAMBDA_MAX - LAMBDA_MIN) / 4.0;
    let want = [0.1, 0.35, 0.6, 0.85].map(|u| LAMBDA_MIN + u * (LAMBDA_MAX - LAMBDA_MIN));
    for (i, want) in want.iter().enumerate() {
        assert!((wl.lambda(i) - want).abs() < 1e-3);
    }
    let wl = SampledWavelengths::sample_from(0.9, WavelengthDistribution::Uniform);
    assert!((wl.lambda(1) - (LAMBDA_MIN + 0.15 * (LAMBDA_MAX - LAMBDA_MIN))).abs() < 1e-3, "wraps: {wl:?}");
    assert!((wl.lambda(2) - wl.lambda(1) - step).abs() < 1e-3);
    // Visible: the same rotation in the distribution's CDF.
    let wl = SampledWavelengths::sample_from(0.6, WavelengthDistribution::Visible);
    let other = SampledWavelengths::sample_from(0.85, WavelengthDistribution::Visible);
    assert_eq!(wl.lambda(1), other.lambda(0));
    for i in 0..4 {
        assert_eq!(wl.pdf()[i], visible_pdf(wl.lambda(i)));
    }
}

/// Issue 31's furnace criterion at the spectral level: the colour of D65 (an RGB white light,
/// which the renderer's illuminant convention turns into D65 times 1) estimated from random
/// wavelengths converges to white within 0.5% chromaticity, and to sRGB (1, 1, 1), with either
/// distribution.
#[test]
fn white_light_converges_to_white() {
    for distribution in [WavelengthDistribution::Visible, WavelengthDistribution::Uniform] {
        let (mean, _) = estimate(200_000, distribution, d65_light, false);
        let c = Color::new(mean[0] as f32, mean[1] as f32, mean[2] as f32);
        let err = chromaticity_error(c);
        assert!(err < 0.005, "{distribution:?}: {c} chromaticity error {err}");
        assert!(mean.iter().all(|m| (m - 1.0).abs() < 0.005), "{distribution:?}: {c}");
    }
}

/// Keeping only the hero (dispersive interfaces) leaves the expected colour unchanged, for a
/// spectrum that varies with wavelength; it is noisier, as it should be.
#[test]
fn terminating_secondary_wavelengths_stays_unbiased() {
    let ramp = |wl: &SampledWavelengths| wl.map(|l| d65(l) * (l - 300.0) / 300.0);
    let (all, sd_all) = estimate(400_000, WavelengthDistribution::Visible, ramp, false);
    let (hero, sd_hero) = estimate(400_000, WavelengthDistribution::Visible, ramp, true);
    for k in 0..3 {
        let tolerance = 4.0 * (sd_all[k].powi(2) + sd_hero[k].powi(2)).sqrt() / 400_000f64.sqrt();
        assert!((all[k] - hero[k]).abs() < tolerance, "channel {k}: {all:?} vs {hero:?}");
        assert!(sd_hero[k] > sd_all[k]);
    }
    let mut wl = SampledWavelengths::sample(0.3);
    let hero_pdf = wl.pdf()[0];
    wl.terminate_secondary();
    assert!(wl.secondary_terminated());
    wl.terminate_secondary();
    assert_eq!(wl.pdf().to_array(), [hero_pdf / 4.0, 0.0, 0.0, 0.0]);
}

/// The measurement behind the default distribution: the per-path standard deviation of a white
/// furnace's colour (D65 light), and of a grey-green reflectance under it, with each.
#[test]
fn visible_sampling_is_less_noisy_than_uniform() {
    let tinted = |wl: &SampledWavelengths| wl.map(|l| d65(l) * (0.3 + 0.5 * (-((l - 530.0) / 60.0).powi(2)).exp()));
    for (name, spectrum) in
        [("white", &d65_light as &dyn Fn(&SampledWavelengths) -> SpectrumSample), ("tinted", &tinted)]
    {
        let (_, visible) = estimate(100_000, WavelengthDistribution::Visible, spectrum, false);
        let (_, uniform) = estimate(100_000, WavelengthDistribution::Uniform, spectrum, false);
        eprintln!("{name}: per-path sRGB standard deviation, visible {visible:.3?}, uniform {uniform:.3?}");
        for k in 0..3 {
            assert!(visible[k] < 0.85 * uniform[k], "{name} channel {k}: {visible:?} vs {uniform:?}");
        }
    }
}

#[test]
fn conversion_uses_the_cie_tables() {
    // At a table sample, the matching functions are the table's values.
    let [x, y, z] = cie_xyz(555.0);
    assert_eq!(
        (x as f64, y as f64, z as f64),
        (CIE_X[39] as f32 as f64, CIE_Y[39] as f32 as f64, CIE_Z[39] as f32 as f64)
    );
    assert_eq!(cie_xyz(359.0), [0.0; 3]);
    assert_eq!(d65(831.0), 0.0);
    // D65's chromaticity is the sRGB white point (0.3127, 0.3290) to 3 digits.
    let (mut sx, mut sy, mut sz) = (0.0, 0.0, 0.0);
    for i in 0..=470 {
        let l = 360.0 + i as f32;
        let [x, y, z] = cie_xyz(l);
        let d = d65(l);
        (sx, sy, sz) = (sx + x * d, sy + y * d, sz + z * d);
    }
    let sum = sx + sy + sz;
    assert!((sx / sum - 0.3127).abs() < 5e-4 && (sy / sum - 0.3290).abs() < 5e-4);
}
