//! `<spectrum>` values as Mitsuba's RGB variants read them: one number, wavelength:value pairs,
//! an `.spd` file, or a spectrum plugin (`uniform`, `regular`, `irregular`, `srgb`, `d65`,
//! `blackbody`), each becoming one linear sRGB colour (see `crate::spectrum`).

use super::Build;
use super::plugins::PluginKind;
use super::props::Cx;
use super::xml::El;
use crate::material::SpectrumId;
use crate::math::Color;
use crate::scene::{FileKind, SceneError};
use crate::spectrum::{CIE_MAX, CIE_MIN, SampledSpectrum, SpectrumUse, equal_energy_white, parse_spd};
use std::ops::Range;

impl<'a> Cx<'a> {
    /// The colour of a `<spectrum>` element for property `name`. A spectrum given as a
    /// spectrum (a constant, a list, a file, `uniform`, `regular`, `irregular`, `blackbody`:
    /// all but `srgb` and `d65`) is also kept in `given_spectrum`, for an emitter or a BSDF to
    /// take.
    pub(super) fn spectrum_color(&mut self, el: &'a El, name: &str, usage: SpectrumUse) -> Result<Color, SceneError> {
        self.given_spectrum = None;
        self.spectrum_color_of(el, name, usage)
    }

    /// The spectrum the colour `color` just read was given as, kept in the scene's table of
    /// reflectance-like spectra for spectral mode (none when it was not given as a spectrum,
    /// or the colour is black).
    pub(super) fn given_id(&mut self, b: &mut Build, color: Color) -> SpectrumId {
        let spectrum = self.given_spectrum.take();
        b.geometry.keep_given_spectrum(spectrum.as_ref(), color)
    }

    /// The colour of an emitter's property `name` and, when it was given as a spectrum, that
    /// spectrum (for spectral mode).
    pub(super) fn emission_color(
        &mut self,
        p: &super::props::Props<'a>,
        name: &str,
    ) -> Result<(Option<Color>, Option<SampledSpectrum>), SceneError> {
        self.given_spectrum = None;
        let color = self.color_for(p, name, SpectrumUse::Emission)?;
        Ok((color, self.given_spectrum.take()))
    }

    fn spectrum_color_of(&mut self, el: &'a El, name: &str, usage: SpectrumUse) -> Result<Color, SceneError> {
        if self.attr(el, "type")?.is_some() {
            return self.spectrum_plugin(el, usage);
        }
        match (self.attr(el, "value")?, self.attr(el, "filename")?) {
            (Some((v, span)), None) => self.spectrum_value(el, name, &v, span, usage),
            (None, Some((f, span))) => self.spectrum_file(el, &f, span, usage),
            (Some(_), Some((_, span))) => {
                Err(self.err_span(el, span, format!("<spectrum> `{name}` takes `value` or `filename`, not both")))
            }
            (None, None) => Err(self.err(el, format!("<spectrum> `{name}` needs `value` or `filename`"))),
        }
    }

    /// `value="0.5"` (a flat spectrum) or `value="400:0.1, 500:0.3, ..."`.
    fn spectrum_value(
        &mut self,
        el: &El,
        name: &str,
        v: &str,
        span: Range<usize>,
        usage: SpectrumUse,
    ) -> Result<Color, SceneError> {
        let tokens: Vec<&str> = v.split(|c: char| c == ',' || c.is_whitespace()).filter(|t| !t.is_empty()).collect();
        if let [one] = tokens.as_slice()
            && !one.contains(':')
        {
            let x = self.parse_f32(el, one, span)?;
            self.given_spectrum = Some(flat(x));
            // A flat emission spectrum is an equal-energy white, which sRGB shows slightly
            // purple; a flat reflectance is grey.
            return Ok(match usage {
                SpectrumUse::Emission => equal_energy_white() * x,
                _ => Color::splat(x),
            });
        }
        let (mut wavelengths, mut values) = (Vec::new(), Vec::new());
        for t in &tokens {
            let Some((w, x)) = t.split_once(':') else {
                return Err(self.err_span(
                    el,
                    span,
                    format!("<spectrum> `{name}` needs one value or wavelength:value pairs, found `{t}`"),
                ));
            };
            wavelengths.push(self.parse_f32(el, w, span.clone())? as f64);
            values.push(self.parse_f32(el, x, span.clone())? as f64);
        }
        let s = SampledSpectrum::new(wavelengths, values).map_err(|m| self.err_span(el, span, m))?;
        self.spectrum_to_color(el, &s, usage)
    }

    /// `filename="x.spd"`, found as Mitsuba finds it while parsing: through the resolver of the
    /// file the element is in.
    fn spectrum_file(
        &mut self,
        el: &El,
        file: &str,
        span: Range<usize>,
        usage: SpectrumUse,
    ) -> Result<Color, SceneError> {
        let resolver = &self.src(el).resolver;
        let Some(path) = resolver.resolve(file).filter(|p| p.is_file()) else {
            let message = format!("spectrum file `{file}` not found (looked in {})", resolver.searched());
            return Err(self.err_span(el, span, message));
        };
        self.files.open(&path, FileKind::Spectrum)?;
        let text = std::fs::read_to_string(&path).map_err(|e| {
            self.err_span(el, span.clone(), format!("cannot read spectrum file `{}`: {e}", path.display()))
        })?;
        let s = parse_spd(&text)
            .map_err(|e| self.err_span(el, span, format!("spectrum file `{}`: {e}", path.display())))?;
        self.spectrum_to_color(el, &s, usage)
    }

    /// `<spectrum type="..." name="...">` with the plugin's own properties.
    fn spectrum_plugin(&mut self, el: &'a El, usage: SpectrumUse) -> Result<Color, SceneError> {
        let p = self.props(el)?;
        let color = match p.kind.as_str() {
            "uniform" => {
                let x = self.float(&p, "value")?.unwrap_or(1.0);
                self.given_spectrum = Some(flat(x));
                Color::splat(x)
            }
            "srgb" | "d65" => {
                let c = match self.prop(&p, "color") {
                    Some(c) => self.color_of_for(c, "color", SpectrumUse::Unbounded)?,
                    None => Color::ONE,
                };
                // An RGB colour: spectral mode lifts it (times D65 on an emitter, as Mitsuba).
                self.given_spectrum = None;
                c * self.float(&p, "scale")?.unwrap_or(1.0)
            }
            "regular" => {
                let min = self.float(&p, "wavelength_min")?.unwrap_or(CIE_MIN as f32) as f64;
                let max = self.float(&p, "wavelength_max")?.unwrap_or(CIE_MAX as f32) as f64;
                let values = self.number_list(&p, "values")?;
                let s = SampledSpectrum::regular(min, max, values).map_err(|m| self.err(el, m))?;
                self.spectrum_to_color(el, &s, usage)?
            }
            "irregular" => {
                let wavelengths = self.number_list(&p, "wavelengths")?;
                let values = self.number_list(&p, "values")?;
                let s = SampledSpectrum::new(wavelengths, values).map_err(|m| self.err(el, m))?;
                self.spectrum_to_color(el, &s, usage)?
            }
            // Mitsuba's RGB variants refuse black bodies; its spectral ones integrate Planck's
            // law against the sensor's matching functions, which is what this colour is.
            "blackbody" => {
                let Some(t) = self.float(&p, "temperature")? else {
                    return Err(self.err(el, "a blackbody spectrum needs <float name=\"temperature\" .../> (kelvin)"));
                };
                let min = self.float(&p, "lambda_min")?.unwrap_or(CIE_MIN as f32) as f64;
                let max = self.float(&p, "lambda_max")?.unwrap_or(CIE_MAX as f32) as f64;
                let s = SampledSpectrum::blackbody(t as f64, min, max).map_err(|m| self.err(el, m))?;
                self.spectrum_to_color(el, &s, usage)?
            }
            other => {
                self.unsupported(el, PluginKind::Spectrum, other, ": it is taken as grey 0.5")?;
                for u in &p.used {
                    u.set(true);
                }
                Color::splat(0.5)
            }
        };
        self.finish(&p)?;
        Ok(color)
    }

    /// A `<string>` of numbers separated by commas or spaces (a spectrum plugin's list).
    fn number_list(&self, p: &super::props::Props<'a>, name: &str) -> Result<Vec<f64>, SceneError> {
        let Some((v, el)) = self.string(p, name)? else {
            return Err(self.err(p.el, format!("a `{}` spectrum needs <string name=\"{name}\" .../>", p.kind)));
        };
        let span = self.value(el)?.1;
        Ok(self.parse_list(el, &v, span)?.into_iter().map(f64::from).collect())
    }

    /// The spectrum's colour, with Mitsuba's warning when it is out of gamut and clamped.
    fn spectrum_to_color(&mut self, el: &El, s: &SampledSpectrum, usage: SpectrumUse) -> Result<Color, SceneError> {
        self.given_spectrum = Some(s.clone());
        let (c, clamped) = s.to_srgb(usage);
        if !c.is_finite() {
            return Err(self.err(el, format!("the spectrum's values are too large for a colour (it gives {c})")));
        }
        if clamped {
            // What Mitsuba does too, so not an error with --strict.
            self.note(el, format!("the spectrum is outside the sRGB gamut here and is clamped to {c}"));
        }
        Ok(c)
    }
}

/// A constant spectrum over the visible range (where spectral mode samples wavelengths).
fn flat(x: f32) -> SampledSpectrum {
    SampledSpectrum::new(vec![CIE_MIN, CIE_MAX], vec![x as f64; 2]).expect("two increasing wavelengths")
}
