//! A smooth dielectric interface (Mitsuba 3's `dielectric`, the seed report's Fresnel glass):
//! reflection and refraction weighted by the Fresnel equations (seed eq. 5-8), total internal
//! reflection included. `uc` chooses reflection with probability F, refraction otherwise.

use super::{BxdfSample, Lobe, LobeFlags, Transport, colour_weight, reflect_local, refract_local};
use crate::material::fresnel::fresnel_dielectric;
use crate::math::{Color, Vec2, Vec3};

/// Glass of relative index `eta` (the index of the side `wi` enters over the side of `wo`);
/// `r` and `t` scale reflection and refraction (Mitsuba's `specular_reflectance` and
/// `specular_transmittance`, 1 for glass). Two delta lobes in one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dielectric {
    pub eta: f32,
    pub r: Color,
    pub t: Color,
}

impl Dielectric {
    /// Clear glass of relative index `eta`.
    pub fn clear(eta: f32) -> Self {
        Dielectric { eta, r: Color::ONE, t: Color::ONE }
    }
}

impl Lobe for Dielectric {
    #[inline]
    fn lifted(self, wl: &crate::spectrum::Wavelengths, eta_ratio: f32) -> Self {
        Dielectric { eta: self.eta * eta_ratio, r: wl.reflectance(self.r), t: wl.reflectance(self.t) }
    }

    #[inline]
    fn flags(&self) -> LobeFlags {
        LobeFlags::SPECULAR_REFLECTION | LobeFlags::SPECULAR_TRANSMISSION
    }

    #[inline]
    fn is_isotropic(&self) -> bool {
        true
    }

    /// 1 for clear glass, which always reflects or transmits everything.
    #[inline]
    fn sampling_weight(&self) -> f32 {
        colour_weight(self.r.max(self.t))
    }

    #[inline]
    fn mean_albedo(&self) -> f32 {
        self.r.max(self.t).mean()
    }

    #[inline]
    fn lambert_albedo(&self) -> Option<Color> {
        None
    }

    #[inline]
    fn scaled(self, w: f32) -> Self {
        let c = Color::splat(w);
        Dielectric { r: self.r * c, t: self.t * c, ..self }
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
    fn sample(&self, wo: Vec3, uc: f32, _u: Vec2, mode: Transport) -> Option<BxdfSample> {
        let fr = fresnel_dielectric(wo.z, self.eta);
        if uc < fr {
            let wi = reflect_local(wo);
            Some(BxdfSample { wi, weight: self.r, pdf: fr, flags: LobeFlags::SPECULAR_REFLECTION })
        } else {
            let wi = refract_local(wo, self.eta)?;
            let scale = if mode == Transport::Radiance { 1.0 / (self.eta * self.eta) } else { 1.0 };
            Some(BxdfSample { wi, weight: self.t * scale, pdf: 1.0 - fr, flags: LobeFlags::SPECULAR_TRANSMISSION })
        }
    }
}
