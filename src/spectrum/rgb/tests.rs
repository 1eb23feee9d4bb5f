use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg32;

use super::*;
use crate::spectrum::sampled::{cie_xyz, xyz_to_color};

/// The colour of `spectrum` (a reflectance, seen under D65) integrated deterministically: the
/// trapezoid rule at 0.5 nm over the CIE tables, independent of the fit's own 1 nm weights.
fn reflectance_colour(spectrum: impl Fn(f32) -> f32) -> [f64; 3] {
    let mut xyz = [0.0f64; 3];
    for i in 0..=940 {
        let l = LAMBDA_MIN + i as f32 * 0.5;
        let w = if i == 0 || i == 940 { 0.25 } else { 0.5 };
        let bar = cie_xyz(l);
        for k in 0..3 {
            xyz[k] += w * (spectrum(l) * d65(l)) as f64 * bar[k] as f64;
        }
    }
    let c = xyz_to_color(xyz.map(|v| (v * CIE_Y_NORMALIZATION) as f32));
    c.to_array().map(f64::from)
}

fn test_colours() -> Vec<[f32; 3]> {
    let mut colours = vec![
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 1.0],
        [1.0, 0.0, 1.0],
        [0.0, 0.0, 0.0],
        [0.18, 0.18, 0.18],
        [0.5, 0.5, 0.5],
        [1.0, 1.0, 1.0],
        [1e-4, 2e-4, 5e-5],
        [3e-3, 1e-3, 2e-3],
        [0.02, 0.0, 0.01],
        [0.999, 0.995, 1.0],
        [0.99, 0.97, 0.98],
        [0.998, 0.92, 0.98],
        [0.95, 0.9, 0.99],
    ];
    let mut rng = Pcg32::seed_from_u64(31);
    colours.extend((0..500).map(|_| [rng.random::<f32>(), rng.random::<f32>(), rng.random::<f32>()]));
    colours
}

fn max_error(a: [f64; 3], b: [f32; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k] as f64).abs()).fold(0.0, f64::max)
}

/// Issue 31's acceptance item: uplifting an sRGB colour and converting it back reproduces it
/// within 1e-3, for random colours, primaries, greys, near-black and near-white; and the
/// spectrum stays within [0, 1].
#[test]
fn albedo_round_trip_within_1e_3() {
    let colours = test_colours();
    let start = std::time::Instant::now();
    let spectra: Vec<RgbAlbedoSpectrum> =
        colours.iter().map(|&c| RgbAlbedoSpectrum::new(Color::from_array(c))).collect();
    eprintln!("albedo fit: {:.1} us per colour", start.elapsed().as_secs_f64() * 1e6 / colours.len() as f64);
    let mut worst = (0.0, [0.0; 3]);
    let mut worst_reachable = 0.0f64;
    for (&rgb, s) in colours.iter().zip(&spectra) {
        let back = reflectance_colour(|l| s.eval(l));
        let e = max_error(back, rgb);
        if e > worst.0 {
            worst = (e, rgb);
        }
        if rgb != [0.999, 0.995, 1.0] {
            worst_reachable = worst_reachable.max(e);
        }
        for i in 0..=470 {
            let v = s.eval(LAMBDA_MIN + i as f32);
            assert!((0.0..=1.0).contains(&v), "{rgb:?}: {v} at {} nm", 360 + i);
        }
    }
    eprintln!("albedo round trip: worst {:.2e} at {:?}; {worst_reachable:.2e} without it", worst.0, worst.1);
    assert!(worst.0 < 1e-3, "worst {:.2e} at {:?}", worst.0, worst.1);
}

/// The table alone (trilinear, as pbrt-v4 and Mitsuba evaluate it): the accuracy the module
/// doc quotes.
#[test]
fn table_lookup_is_close() {
    let mut worst = 0.0f64;
    for rgb in test_colours() {
        let p = SigmoidPolynomial::from_table(rgb);
        worst = worst.max(max_error(reflectance_colour(|l| p.eval(l)), rgb));
    }
    eprintln!("table alone: worst {worst:.2e}");
    assert!(worst < 3e-2, "{worst}");
}

#[test]
fn unbounded_and_illuminant_colours_round_trip() {
    for rgb in [[2.0, 0.5, 0.1], [0.3, 7.0, 1.0], [1.0, 1.0, 1.0], [0.05, 0.02, 0.9], [0.0, 0.0, 0.0]] {
        let s = RgbUnboundedSpectrum::new(Color::from_array(rgb));
        let back = reflectance_colour(|l| s.eval(l));
        let m = rgb.iter().cloned().fold(1.0f32, f32::max) as f64;
        assert!(max_error(back, rgb) < 1e-3 * m, "{rgb:?} -> {back:?}");
        // An illuminant's emission (no further D65) has the same colour.
        let e = RgbIlluminantSpectrum::new(Color::from_array(rgb));
        let emitted = reflectance_colour(|l| if d65(l) > 0.0 { e.eval(l) / d65(l) } else { 0.0 });
        assert!(max_error(emitted, rgb) < 1e-3 * m, "{rgb:?} -> {emitted:?}");
    }
    // RGB white light is D65 itself.
    let white = RgbIlluminantSpectrum::new(Color::ONE);
    for l in [380.0, 455.5, 560.0, 700.0] {
        assert!((white.eval(l) - d65(l)).abs() <= 1e-6 * d65(l));
    }
}

/// Spectral mode's lifts at a path's wavelengths are these spectra's (the table's) values.
#[test]
fn lanes_evaluate_the_table_spectra() {
    let wl = crate::spectrum::Wavelengths::sample(0.37);
    let c = Color::new(0.7, 0.2, 0.4);
    let (s, v) = (RgbAlbedoSpectrum::from_table(c), wl.reflectance(c));
    for i in 0..3 {
        assert!((v[i] - s.eval(wl.lambda(i))).abs() <= 1e-6, "{v:?}");
    }
    let c = Color::new(3.0, 1.0, 0.5);
    let (e, v) = (RgbIlluminantSpectrum::from_table(c), wl.illuminant(c));
    for i in 0..3 {
        assert!((v[i] - e.eval(wl.lambda(i))).abs() <= 1e-5 * v[i].abs(), "{v:?}");
    }
}

#[test]
fn greys_are_exact_constants_and_max_value_bounds() {
    for v in [0.0, 0.25, 0.5, 0.9, 1.0] {
        let p = SigmoidPolynomial::fit([v; 3]);
        for l in [360.0, 500.0, 830.0] {
            assert!((p.eval(l) - v).abs() < 1e-6, "{v}: {}", p.eval(l));
        }
    }
    let p = SigmoidPolynomial::fit([0.1, 0.8, 0.3]);
    let m = p.max_value();
    let sweep = (0..=4700).map(|i| p.eval(360.0 + i as f32 * 0.1)).fold(0.0f32, f32::max);
    assert!(sweep <= m * 1.00001 && sweep >= m * 0.9999, "{sweep} vs {m}");
}

#[test]
fn bad_tables_are_refused() {
    assert_eq!(RgbToSpectrumTable::parse(b"nonsense bytes here").err(), Some(TableError::Magic));
    let mut bytes = TABLE_BYTES.to_vec();
    bytes[8] = 2;
    assert_eq!(RgbToSpectrumTable::parse(&bytes).err(), Some(TableError::Version(2)));
    let short = &TABLE_BYTES[..TABLE_BYTES.len() - 4];
    assert!(matches!(RgbToSpectrumTable::parse(short), Err(TableError::Size { .. })));
    assert_eq!(RgbToSpectrumTable::srgb().resolution(), 32);
}
