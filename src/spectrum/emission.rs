//! Emitted spectra kept as the scene gave them (a Mitsuba `<spectrum>` on an emitter: a
//! wavelength:value list, an `.spd` file, a regular or irregular spectrum, a black body), for
//! spectral mode to evaluate at each path's wavelengths. Lifting the spectrum's sRGB colour back
//! to a smooth spectrum would lose its shape: a sodium lamp's lines, a black body's slope.
//!
//! RGB mode keeps using the colour (`SampledSpectrum::to_srgb`); the light's code computes with
//! that colour as before, scaled by whatever it is scaled by (intensity, a sampling density).
//! So a spectrum stands for its colour `rgb`, and spectral mode turns an emitted colour `le` of
//! the light into the spectrum times le / rgb, read in the colour's largest channel.

use super::SampledSpectrum;
use super::lanes::Wavelengths;
use crate::math::Color;

/// A piecewise-linear emitted spectrum (zero outside its wavelengths, as Mitsuba's) and the
/// colour it stands for in RGB mode.
#[derive(Clone, Debug, PartialEq)]
pub struct EmissionSpectrum {
    lambda: Vec<f32>,
    values: Vec<f32>,
    /// The colour's largest channel and one over its value there.
    channel: usize,
    inv: f32,
}

impl EmissionSpectrum {
    /// `s`, standing for colour `rgb`; `None` when the colour is black (nothing to scale by).
    pub fn new(s: &SampledSpectrum, rgb: Color) -> Option<Self> {
        let channel = (0..3).max_by(|&a, &b| rgb[a].total_cmp(&rgb[b]))?;
        if !(rgb[channel] > 0.0 && rgb[channel].is_finite()) {
            return None;
        }
        Some(EmissionSpectrum {
            lambda: s.wavelengths().iter().map(|&l| l as f32).collect(),
            values: s.values().iter().map(|&v| v as f32).collect(),
            channel,
            inv: 1.0 / rgb[channel],
        })
    }

    /// The value at `w` nm: linear between samples, zero outside them.
    #[inline]
    pub fn eval(&self, w: f32) -> f32 {
        let (l, v) = (&self.lambda, &self.values);
        let last = l.len() - 1;
        if !(w >= l[0] && w <= l[last]) {
            return 0.0;
        }
        let i = l.partition_point(|&x| x <= w).saturating_sub(1).min(last - 1);
        let t = (w - l[i]) / (l[i + 1] - l[i]);
        v[i] + (v[i + 1] - v[i]) * t
    }

    /// The light's emitted colour `le` (its colour times a factor) as this spectrum at the
    /// lanes' wavelengths, times the same factor.
    #[inline]
    pub fn at(&self, le: Color, wl: &Wavelengths) -> Color {
        let factor = le[self.channel] * self.inv;
        if factor == 0.0 {
            return Color::ZERO;
        }
        wl.map(|l| self.eval(l)) * factor
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scales_with_the_colour_and_interpolates() {
        let s = SampledSpectrum::new(vec![500.0, 600.0], vec![2.0, 4.0]).unwrap();
        let rgb = Color::new(0.5, 2.0, 1.0);
        let e = EmissionSpectrum::new(&s, rgb).unwrap();
        let wl = Wavelengths::single(550.0);
        // Twice the light's colour: twice its spectrum.
        assert_eq!(e.at(rgb * 2.0, &wl), Color::splat(6.0));
        assert_eq!(e.eval(499.0), 0.0);
        assert_eq!(e.eval(601.0), 0.0);
        assert_eq!(e.eval(600.0), 4.0);
        assert!(EmissionSpectrum::new(&s, Color::ZERO).is_none());
    }
}
