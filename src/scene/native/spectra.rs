//! Spectra written in TOML scenes where a colour may be (`de::SpectrumSpec`): read into the
//! sampled spectrum spectral mode evaluates as given, and the colour RGB mode renders (what
//! Mitsuba's RGB variants make of the same spectrum).

use super::Cx;
use crate::material::{GivenSpectra, SpectrumId};
use crate::math::Color;
use crate::scene::SceneError;
use crate::scene::builder::SceneBuilder;
use crate::scene::de::{ColorSpec, SpectrumSpec};
use crate::scene::footprint::FileKind;
use crate::spectrum::{CIE_MAX, CIE_MIN, SampledSpectrum, SpectrumUse, parse_spd};
use std::ops::Range;
use toml::Spanned;

/// The spectra written for a plain material's constant colours, in `GivenSpectra::colors`'
/// order, with the colours they stand for; added to the scene once the material has its index.
pub(super) type MaterialSpectra = [Option<(SampledSpectrum, Color)>; 2];

impl Cx<'_> {
    /// `spec` as a sampled spectrum and its colour for `usage`.
    pub(super) fn spectrum(
        &self,
        spec: &SpectrumSpec,
        usage: SpectrumUse,
        span: Range<usize>,
    ) -> Result<(Color, SampledSpectrum), SceneError> {
        let s = match spec {
            SpectrumSpec::Samples(pairs) => {
                SampledSpectrum::new(pairs.iter().map(|p| p.0).collect(), pairs.iter().map(|p| p.1).collect())
            }
            SpectrumSpec::File(file) => {
                let path = self.base.join(file);
                if !path.is_file() {
                    return Err(self.at(span, format!("spectrum file `{}` not found", path.display())));
                }
                self.files.open(&path, FileKind::Spectrum)?;
                let text = std::fs::read_to_string(&path).map_err(|e| {
                    self.at(span.clone(), format!("cannot read spectrum file `{}`: {e}", path.display()))
                })?;
                parse_spd(&text).map_err(|e| format!("spectrum file `{}`: {e}", path.display()))
            }
            SpectrumSpec::Blackbody(kelvin) => SampledSpectrum::blackbody(*kelvin, CIE_MIN, CIE_MAX),
        }
        .map_err(|m| self.at(span.clone(), m))?;
        let (color, _) = s.to_srgb(usage);
        if !color.is_finite() {
            return Err(self.at(span, format!("the spectrum's values are too large for a colour (it gives {color})")));
        }
        Ok((color, s))
    }

    /// An emitted colour (a light's `color`, an object's `emission`) and its spectrum when it was
    /// written as one.
    pub(super) fn emitted(
        &self,
        c: Option<&Spanned<ColorSpec>>,
    ) -> Result<(Option<Color>, Option<SampledSpectrum>), SceneError> {
        match c.map(|c| (c.get_ref(), c.span())) {
            None => Ok((None, None)),
            Some((ColorSpec::Rgb(c), _)) => Ok((Some(*c), None)),
            Some((ColorSpec::Spectrum(s), span)) => {
                let (c, s) = self.spectrum(s, SpectrumUse::Emission, span)?;
                Ok((Some(c), Some(s)))
            }
        }
    }
}

/// Spectral mode evaluates `spectra` for material `m`'s constant colours.
pub(super) fn keep_material(geometry: &mut SceneBuilder, m: u32, spectra: MaterialSpectra) {
    let mut given = GivenSpectra::NONE;
    for (id, s) in given.colors.iter_mut().zip(spectra) {
        *id = s.map_or(SpectrumId::NONE, |(s, c)| geometry.keep_given_spectrum(Some(&s), c));
    }
    geometry.set_material_spectra(m, given);
}
