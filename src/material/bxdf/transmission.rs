//! Perfect refraction with a fixed transmittance (seed eq. 4, the seed report's `transparent`
//! k_t): no Fresnel weighting, and under total internal reflection the share that cannot leave
//! is reflected, as the Whitted integrator (and the seed report's fix for its image 5) does.

use super::{BxdfSample, Lobe, LobeFlags, Transport, reflect_local, refract_local};
use crate::math::{Color, Vec2, Vec3};

/// Refraction with transmittance `t`; `eta` is the index of the side `wi` enters over the side
/// of `wo`. A delta lobe.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transmission {
    pub t: f32,
    pub eta: f32,
}

impl Lobe for Transmission {
    #[inline]
    fn lifted(self, _wl: &crate::spectrum::Wavelengths, eta_ratio: f32) -> Self {
        Transmission { eta: self.eta * eta_ratio, ..self }
    }

    #[inline]
    fn flags(&self) -> LobeFlags {
        LobeFlags::SPECULAR_TRANSMISSION
    }

    #[inline]
    fn is_isotropic(&self) -> bool {
        true
    }

    #[inline]
    fn sampling_weight(&self) -> f32 {
        self.t
    }

    #[inline]
    fn mean_albedo(&self) -> f32 {
        self.t
    }

    #[inline]
    fn lambert_albedo(&self) -> Option<Color> {
        None
    }

    #[inline]
    fn scaled(self, w: f32) -> Self {
        Transmission { t: self.t * w, ..self }
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
    fn sample(&self, wo: Vec3, _uc: f32, _u: Vec2, mode: Transport) -> Option<BxdfSample> {
        match refract_local(wo, self.eta) {
            Some(wi) => {
                let scale = if mode == Transport::Radiance { 1.0 / (self.eta * self.eta) } else { 1.0 };
                Some(BxdfSample {
                    wi,
                    weight: Color::splat(self.t * scale),
                    pdf: 1.0,
                    flags: LobeFlags::SPECULAR_TRANSMISSION,
                })
            }
            None => Some(BxdfSample {
                wi: reflect_local(wo),
                weight: Color::splat(self.t),
                pdf: 1.0,
                flags: LobeFlags::SPECULAR_REFLECTION,
            }),
        }
    }
}
