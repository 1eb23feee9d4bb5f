//! A smooth metal (Mitsuba 3's `conductor`): a mirror tinted by the complex Fresnel reflectance.
//! It reflects only on the side the normal faces.

use super::{BxdfSample, Lobe, LobeFlags, Transport, colour_weight, reflect_local};
use crate::material::conductors::Measured;
use crate::material::fresnel::fresnel_conductor_rgb;
use crate::math::{Color, Vec2, Vec3};

/// Mirror reflection weighted by the conductor Fresnel term of complex index `eta` + i `k` (per
/// RGB channel), times `scale` (Mitsuba's `specular_reflectance`). A delta lobe.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conductor {
    pub eta: Color,
    pub k: Color,
    /// A named metal's measured spectra, which spectral mode evaluates instead of lifting
    /// `eta` and `k`.
    pub measured: Option<Measured>,
    pub scale: Color,
}

impl Conductor {
    /// Reflectance at normal incidence: the lobe's albedo estimate for sampling.
    #[inline]
    pub fn albedo(&self) -> Color {
        fresnel_conductor_rgb(1.0, self.eta, self.k) * self.scale
    }
}

impl Lobe for Conductor {
    #[inline]
    fn lifted(self, wl: &crate::spectrum::Wavelengths, _eta_ratio: f32) -> Self {
        let (eta, k) = match self.measured {
            Some(m) => m.at(wl),
            None => (wl.unbounded(self.eta), wl.unbounded(self.k)),
        };
        Conductor { eta, k, measured: None, scale: wl.reflectance(self.scale) }
    }

    #[inline]
    fn flags(&self) -> LobeFlags {
        LobeFlags::SPECULAR_REFLECTION
    }

    #[inline]
    fn is_isotropic(&self) -> bool {
        true
    }

    #[inline]
    fn sampling_weight(&self) -> f32 {
        colour_weight(self.albedo())
    }

    #[inline]
    fn mean_albedo(&self) -> f32 {
        self.albedo().mean()
    }

    #[inline]
    fn lambert_albedo(&self) -> Option<Color> {
        None
    }

    #[inline]
    fn scaled(self, w: f32) -> Self {
        Conductor { scale: self.scale * Color::splat(w), ..self }
    }

    #[inline]
    fn f(&self, _wo: Vec3, _wi: Vec3, _mode: Transport) -> Color {
        Color::ZERO
    }

    #[inline]
    fn pdf(&self, _wo: Vec3, _wi: Vec3, _mode: Transport) -> f32 {
        0.0
    }

    #[inline]
    fn sample(&self, wo: Vec3, _uc: f32, _u: Vec2, _mode: Transport) -> Option<BxdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let weight = fresnel_conductor_rgb(wo.z, self.eta, self.k) * self.scale;
        Some(BxdfSample { wi: reflect_local(wo), weight, pdf: 1.0, flags: LobeFlags::SPECULAR_REFLECTION })
    }
}
