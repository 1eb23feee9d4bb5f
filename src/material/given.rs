//! Reflectance-like spectra kept as the scene gave them (a Mitsuba `<spectrum>` list or file as a
//! diffuse reflectance, a specular reflectance or transmittance, a conductor's eta or k), for
//! spectral mode to evaluate at each path's wavelengths: lifting their sRGB colour back to a
//! smooth spectrum would lose a narrow band or a step.
//!
//! RGB mode keeps the colour and never looks here. A spectrum stands for its colour, as an
//! emitted one does (`EmissionSpectrum`): a lobe's colour is that colour times whatever the
//! material did to it linearly (a blend's share, a mask's opacity, the coating's 1 / eta^2), so
//! spectral mode evaluates the spectrum times the same factor. Only constant parameters have
//! spectra; textured ones, the principled models and a nonlinear plastic's base are lifted from
//! their colours as before.

use super::bxdf::Bxdf;
use crate::math::Color;
use crate::spectrum::{EmissionSpectrum, Wavelengths};

/// A spectrum standing for a colour (see the module's comment). The same representation as an
/// emitted spectrum: piecewise linear, zero outside its wavelengths (as Mitsuba's).
pub type GivenSpectrum = EmissionSpectrum;

/// An index into `Materials::spectra`, or none (the colour is lifted).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SpectrumId(u16);

impl SpectrumId {
    pub const NONE: SpectrumId = SpectrumId(u16::MAX);

    /// The `i`th spectrum of the table; none past the index's range (the colour is lifted).
    pub fn new(i: usize) -> Self {
        SpectrumId(u16::try_from(i).ok().filter(|&i| i != u16::MAX).unwrap_or(u16::MAX))
    }

    #[inline]
    pub fn is_none(self) -> bool {
        self == SpectrumId::NONE
    }

    /// The index in the table (meaningless for `NONE`).
    #[inline]
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

impl Default for SpectrumId {
    fn default() -> Self {
        SpectrumId::NONE
    }
}

/// The spectra given for a plain material's constant parameters: its colour parameters in the
/// order `Plain::params` lists them (a diffuse reflectance; a conductor's specular reflectance;
/// a dielectric's reflectance and transmittance; a plastic's diffuse and specular reflectance),
/// and a conductor's eta and k.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GivenSpectra {
    pub colors: [SpectrumId; 2],
    pub eta: SpectrumId,
    pub k: SpectrumId,
}

impl GivenSpectra {
    pub const NONE: GivenSpectra =
        GivenSpectra { colors: [SpectrumId::NONE; 2], eta: SpectrumId::NONE, k: SpectrumId::NONE };

    pub fn is_none(&self) -> bool {
        *self == GivenSpectra::NONE
    }
}

/// The spectra of one lobe's colours: `[0]` its first colour (Lambert `r`, a conductor's or a
/// coating's `scale`, a dielectric's `r`, a plastic base's `d`), `[1]` a dielectric's `t` or a
/// conductor's `eta`, `[2]` a conductor's `k`.
pub type LobeSpectra = [SpectrumId; 3];

pub const NO_LOBE_SPECTRA: LobeSpectra = [SpectrumId::NONE; 3];

/// `lobe` lifted to `wl` (`Bxdf::lifted`), with the colours that have a spectrum in `ids`
/// evaluated from it instead.
#[inline]
pub fn lifted(lobe: Bxdf, ids: &LobeSpectra, table: &[GivenSpectrum], wl: &Wavelengths, eta_ratio: f32) -> Bxdf {
    let lifted = lobe.lifted(wl, eta_ratio);
    if *ids == NO_LOBE_SPECTRA {
        return lifted;
    }
    // The lobe's colour `c` as spectrum `ids[i]`, or its lift `l` without one.
    let at = |i: usize, c: Color, l: Color| match ids[i] {
        SpectrumId(s) if s != u16::MAX => table[s as usize].at(c, wl),
        _ => l,
    };
    match (lobe, lifted) {
        (Bxdf::Lambert(o), Bxdf::Lambert(mut l)) => {
            l.r = at(0, o.r, l.r);
            Bxdf::Lambert(l)
        }
        (Bxdf::Conductor(o), Bxdf::Conductor(mut l)) => {
            l.scale = at(0, o.scale, l.scale);
            l.eta = at(1, o.eta, l.eta);
            l.k = at(2, o.k, l.k);
            Bxdf::Conductor(l)
        }
        (Bxdf::RoughConductor(o), Bxdf::RoughConductor(mut l)) => {
            l.scale = at(0, o.scale, l.scale);
            l.eta = at(1, o.eta, l.eta);
            l.k = at(2, o.k, l.k);
            Bxdf::RoughConductor(l)
        }
        (Bxdf::Dielectric(o), Bxdf::Dielectric(mut l)) => {
            l.r = at(0, o.r, l.r);
            l.t = at(1, o.t, l.t);
            Bxdf::Dielectric(l)
        }
        (Bxdf::RoughDielectric(o), Bxdf::RoughDielectric(mut l)) => {
            l.r = at(0, o.r, l.r);
            l.t = at(1, o.t, l.t);
            Bxdf::RoughDielectric(l)
        }
        (Bxdf::FresnelMirror(o), Bxdf::FresnelMirror(mut l)) => {
            l.scale = at(0, o.scale, l.scale);
            Bxdf::FresnelMirror(l)
        }
        (Bxdf::RoughCoating(o), Bxdf::RoughCoating(mut l)) => {
            l.scale = at(0, o.scale, l.scale);
            Bxdf::RoughCoating(l)
        }
        (Bxdf::PlasticDiffuse(o), Bxdf::PlasticDiffuse(mut l)) => {
            l.d = at(0, o.d, l.d);
            Bxdf::PlasticDiffuse(l)
        }
        (Bxdf::RoughPlasticDiffuse(o), Bxdf::RoughPlasticDiffuse(mut l)) => {
            l.d = at(0, o.d, l.d);
            Bxdf::RoughPlasticDiffuse(l)
        }
        (_, l) => l,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::bsdf::Lobes;
    use crate::material::bxdf::Lambert;
    use crate::spectrum::SampledSpectrum;

    /// A step at 600 nm whose colour is `rgb`: a lobe of that colour, halved by a blend, lifts
    /// to half the step at each wavelength; a lobe without a spectrum keeps the colour's lift.
    #[test]
    fn lobes_evaluate_their_spectra_times_the_materials_factor() {
        let s = SampledSpectrum::new(vec![360.0, 599.0, 601.0, 830.0], vec![0.1, 0.1, 0.8, 0.8]).unwrap();
        let rgb = Color::new(0.6, 0.3, 0.1);
        let table = [GivenSpectrum::new(&s, rgb).unwrap()];
        let mut own = Lobes::default();
        own.add_given(Bxdf::Lambert(Lambert { r: rgb }), [SpectrumId::new(0), SpectrumId::NONE, SpectrumId::NONE]);
        let mut blend = Lobes::default();
        blend.add_scaled(&own, 0.5);
        blend.add(Bxdf::Lambert(Lambert { r: rgb }));
        let wl = Wavelengths::single(500.0);
        let lifted = blend.lifted(&wl, 1.0, &table);
        let [Bxdf::Lambert(a), Bxdf::Lambert(b)] = lifted.as_slice() else { panic!("two Lambert lobes") };
        for (w, v) in [(500.0, 0.05), (700.0, 0.4)] {
            let wl = Wavelengths::single(w);
            let Bxdf::Lambert(l) = blend.lifted(&wl, 1.0, &table).as_slice()[0] else { unreachable!() };
            assert!((l.r[0] - v).abs() < 1e-6, "{w} nm: {}", l.r[0]);
        }
        assert!((a.r[0] - 0.05).abs() < 1e-6);
        assert_eq!(b.r, wl.reflectance(rgb));
    }
}
