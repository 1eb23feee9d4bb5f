//! Spectra given as data (wavelength:value lists, `.spd` files, black bodies) and their colour:
//! turned into linear sRGB as Mitsuba 3's RGB variants turn them, so that a scene written for
//! Mitsuba with spectral inputs renders here in the colours Mitsuba shows.
//!
//! The conversion integrates the piecewise-linear spectrum against the CIE 1931 matching
//! functions at 1000 evenly spaced wavelengths over 360-830 nm (nothing outside the given
//! range), scales by the luminance normalisation and maps XYZ to linear sRGB. Reflectances
//! (and other unitless colours) are first multiplied by the D65 illuminant, so that a flat
//! spectrum of ones is white; emitted spectra are not, so a flat emission spectrum is the
//! slightly purple colour of an equal-energy white in sRGB.
//!
//! Spectral rendering (issue 31): `lanes` (`Wavelengths`, a path's four wavelengths in the
//! lanes of `Color`, the lifts of colours and the conversion back), `sampled` (the CIE tables at
//! any wavelength, the visible-light distribution), `rgb` (RGB colours uplifted to smooth
//! spectra, Jakob and Hanika 2019), `emission` (emitted spectra kept as given), `blackbody` and
//! `dispersion` (indices of refraction over wavelength, named glasses).

mod blackbody;
mod cie_tables;
mod dispersion;
mod emission;
mod lanes;
mod rgb;
mod sampled;
mod spd;

pub use blackbody::{Blackbody, BlackbodyError, WIEN_B};
pub use cie_tables::{CIE_MAX, CIE_MIN, XYZ_TO_SRGB};
pub use dispersion::{Dispersion, DispersionError, LAMBDA_C, LAMBDA_D, LAMBDA_F};
pub use emission::EmissionSpectrum;
pub use lanes::{LANES, Wavelengths, joined};
pub use rgb::{
    RgbAlbedoSpectrum, RgbIlluminantSpectrum, RgbToSpectrumTable, RgbUnboundedSpectrum, SigmoidPolynomial, TableError,
};
pub use sampled::{LAMBDA_MAX, LAMBDA_MIN, cie_xyz, d65, visible_pdf, xyz_to_color};
pub use spd::{SpdError, parse_spd};

use crate::math::Color;
use cie_tables::{CIE_STEP, CIE_X, CIE_Y, CIE_Y_NORMALIZATION, CIE_Z, D65};

/// Number of wavelengths the conversion sums over (Mitsuba's count).
const STEPS: usize = 1000;

/// What a spectrum stands for, which decides how it becomes a colour.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpectrumUse {
    /// A reflectance or transmittance: weighted by D65, clamped to [0, 1].
    Reflectance,
    /// A unitless quantity that may exceed 1 (a conductor's eta and k): weighted by D65,
    /// negative channels clamped to 0.
    Unbounded,
    /// Emitted radiance, intensity or irradiance: not weighted, negative channels clamped.
    Emission,
}

/// A spectrum sampled at increasing wavelengths (nm), linear in between and zero outside.
#[derive(Clone, Debug, PartialEq)]
pub struct SampledSpectrum {
    wavelengths: Vec<f64>,
    values: Vec<f64>,
}

impl SampledSpectrum {
    /// Checks the samples: at least two, finite, wavelengths strictly increasing.
    pub fn new(wavelengths: Vec<f64>, values: Vec<f64>) -> Result<SampledSpectrum, String> {
        if wavelengths.len() != values.len() {
            return Err(format!("{} wavelengths but {} values", wavelengths.len(), values.len()));
        }
        if wavelengths.len() < 2 {
            return Err("a spectrum needs at least two wavelength:value pairs".into());
        }
        if let Some(x) = wavelengths.iter().chain(&values).find(|x| !x.is_finite()) {
            return Err(format!("spectrum samples must be finite numbers, found {x}"));
        }
        if let Some(w) = wavelengths.windows(2).find(|w| w[1] <= w[0]) {
            return Err(format!("wavelengths must increase, but {} follows {}", w[1], w[0]));
        }
        Ok(SampledSpectrum { wavelengths, values })
    }

    /// `n` >= 2 values evenly spaced from `min` to `max` nm (Mitsuba's `regular` spectrum).
    pub fn regular(min: f64, max: f64, values: Vec<f64>) -> Result<SampledSpectrum, String> {
        if values.len() < 2 {
            return Err("a regular spectrum needs at least two values".into());
        }
        let step = (max - min) / (values.len() - 1) as f64;
        let wavelengths = (0..values.len()).map(|i| min + step * i as f64).collect();
        SampledSpectrum::new(wavelengths, values)
    }

    /// Planck's law for a black body at `kelvin`, in W / (m^2 sr nm), sampled every nanometre
    /// over [min, max] nm (Mitsuba's `blackbody` spectrum).
    pub fn blackbody(kelvin: f64, min: f64, max: f64) -> Result<SampledSpectrum, String> {
        if !(kelvin.is_finite() && kelvin > 0.0) {
            return Err(format!("a black body needs a positive temperature in kelvin, found {kelvin}"));
        }
        if !(min.is_finite() && max.is_finite() && min > 0.0 && max > min) {
            return Err(format!(
                "a black body's wavelength range must be 0 < lambda_min < lambda_max, found {min}..{max}"
            ));
        }
        let n = ((max - min).ceil() as usize).clamp(1, 100_000) + 1;
        let step = (max - min) / (n - 1) as f64;
        let wavelengths: Vec<f64> = (0..n).map(|i| min + step * i as f64).collect();
        let values = wavelengths.iter().map(|&l| planck(kelvin, l)).collect();
        SampledSpectrum::new(wavelengths, values)
    }

    pub fn wavelengths(&self) -> &[f64] {
        &self.wavelengths
    }

    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// The value at `w` nm: linear between samples, zero outside them.
    pub fn eval(&self, w: f64) -> f64 {
        let (l, v) = (&self.wavelengths, &self.values);
        if w < l[0] || w > l[l.len() - 1] {
            return 0.0;
        }
        // The last sample whose wavelength is <= w, but at most the second-to-last.
        let i = l.partition_point(|&x| x <= w).saturating_sub(1).min(l.len() - 2);
        let t = (w - l[i]) / (l[i + 1] - l[i]);
        v[i] * (1.0 - t) + v[i + 1] * t
    }

    /// Its colour in linear sRGB, and whether a channel had to be clamped (out of gamut).
    pub fn to_srgb(&self, usage: SpectrumUse) -> (Color, bool) {
        let mut xyz = [0.0f64; 3];
        for i in 0..STEPS {
            let w = CIE_MIN + (i as f64 / (STEPS - 1) as f64) * (CIE_MAX - CIE_MIN);
            if w < self.wavelengths[0] || w > self.wavelengths[self.wavelengths.len() - 1] {
                continue;
            }
            let mut v = self.eval(w);
            if usage != SpectrumUse::Emission {
                v *= table(&D65, w);
            }
            xyz[0] += table(&CIE_X, w) * v;
            xyz[1] += table(&CIE_Y, w) * v;
            xyz[2] += table(&CIE_Z, w) * v;
        }
        let scale = (CIE_MAX - CIE_MIN) / STEPS as f64 * CIE_Y_NORMALIZATION;
        let rgb = xyz_to_srgb(xyz.map(|c| c * scale));
        let clamped = rgb.map(|c| match usage {
            SpectrumUse::Reflectance => c.clamp(0.0, 1.0),
            _ => c.max(0.0),
        });
        let out_of_gamut = clamped != rgb;
        (Color::new(clamped[0] as f32, clamped[1] as f32, clamped[2] as f32), out_of_gamut)
    }
}

/// The colour Mitsuba's RGB variants give a flat emission spectrum of 1 (an equal-energy white
/// seen in sRGB, whose white is D65): a uniform `<spectrum>` on an emitter is this times its
/// value.
pub fn equal_energy_white() -> Color {
    let c = xyz_to_srgb([1.0, 1.0, 1.0]);
    Color::new(c[0] as f32, c[1] as f32, c[2] as f32)
}

/// Spectral radiance of a black body at `kelvin`, W / (m^2 sr nm), at `nm` nanometres.
pub fn planck(kelvin: f64, nm: f64) -> f64 {
    // CODATA 2014 constants, as Mitsuba uses them.
    const C: f64 = 2.997_924_58e8;
    const H: f64 = 6.626_070_04e-34;
    const K: f64 = 1.380_648_52e-23;
    let l = nm * 1e-9;
    // Per metre of wavelength, then per nanometre.
    1e-9 * 2.0 * H * C * C / (l.powi(5) * ((H * C / (K * l * kelvin)).exp() - 1.0))
}

fn xyz_to_srgb(xyz: [f64; 3]) -> [f64; 3] {
    XYZ_TO_SRGB.map(|row| row[0] * xyz[0] + row[1] * xyz[1] + row[2] * xyz[2])
}

/// A 5 nm CIE table at `w` nm, linearly interpolated (zero outside the table).
fn table(t: &[f64], w: f64) -> f64 {
    let x = (w - CIE_MIN) / CIE_STEP;
    if !(0.0..=(t.len() - 1) as f64).contains(&x) {
        return 0.0;
    }
    let i = (x as usize).min(t.len() - 2);
    let f = x - i as f64;
    t[i] * (1.0 - f) + t[i + 1] * f
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Values printed by Mitsuba 3.9.1's `mi.spectrum_list_to_srgb` (scalar_rgb) for the same
    /// lists (bounded and d65 as the parser sets them per use).
    #[test]
    fn colours_match_mitsubas_conversion() {
        let ramp = SampledSpectrum::new(vec![400.0, 500.0, 600.0, 700.0], vec![0.0, 8.0, 15.6, 18.4]).unwrap();
        let cases = [
            (&ramp, SpectrumUse::Emission, [20.7108, 10.8546, 2.77115]),
            (&ramp, SpectrumUse::Unbounded, [17.7147, 11.3544, 3.30451]),
            (&ramp, SpectrumUse::Reflectance, [1.0, 1.0, 1.0]),
        ];
        for (s, usage, want) in cases {
            let (c, _) = s.to_srgb(usage);
            for k in 0..3 {
                assert!((c[k] as f64 / want[k] - 1.0).abs() < 2e-4, "{usage:?}: {c} vs {want:?}");
            }
        }
        let flat = SampledSpectrum::new(vec![360.0, 830.0], vec![1.0, 1.0]).unwrap();
        let (c, clamped) = flat.to_srgb(SpectrumUse::Emission);
        for (k, want) in [1.20488, 0.948229, 0.909267].into_iter().enumerate() {
            assert!((c[k] as f64 / want - 1.0).abs() < 2e-4, "flat emission {c}");
        }
        assert!(!clamped);
        let (c, _) = flat.to_srgb(SpectrumUse::Unbounded);
        for k in 0..3 {
            assert!((c[k] as f64 / 0.99888 - 1.0).abs() < 2e-4, "flat reflectance {c}");
        }
    }

    #[test]
    fn interpolation_is_linear_and_zero_outside() {
        let s = SampledSpectrum::new(vec![400.0, 500.0, 700.0], vec![1.0, 3.0, 0.0]).unwrap();
        assert_eq!(s.eval(399.9), 0.0);
        assert_eq!(s.eval(700.1), 0.0);
        assert!((s.eval(450.0) - 2.0).abs() < 1e-12);
        assert!((s.eval(600.0) - 1.5).abs() < 1e-12);
        assert!((s.eval(700.0) - 0.0).abs() < 1e-12);
        assert!(SampledSpectrum::new(vec![400.0, 400.0], vec![1.0, 1.0]).is_err());
        assert!(SampledSpectrum::new(vec![400.0], vec![1.0]).is_err());
        assert!(SampledSpectrum::new(vec![400.0, f64::NAN], vec![1.0, 1.0]).is_err());
    }

    /// Wien's displacement law: the peak of Planck's law is at b / T (b = 2.897771955e-3 m K),
    /// and the Stefan-Boltzmann law: pi times the radiance integrated over all wavelengths is
    /// sigma T^4.
    #[test]
    fn planck_peaks_where_wien_says_and_integrates_to_stefan_boltzmann() {
        let t = 5000.0;
        let peak = (100..4000).map(|i| i as f64).max_by(|a, b| planck(t, *a).total_cmp(&planck(t, *b))).unwrap();
        assert!((peak - 2.897771955e6 / t).abs() <= 1.0, "peak at {peak} nm");
        let total: f64 = (1..200_000).map(|i| planck(t, i as f64 * 0.5) * 0.5).sum();
        let sigma = 5.670367e-8;
        assert!((std::f64::consts::PI * total / (sigma * t.powi(4)) - 1.0).abs() < 1e-3);
    }
}
