//! A smooth plastic's base (Mitsuba 3's `plastic`), seen through the coating: the diffuse light
//! enters and leaves through the coating (its transmittance both ways and 1 / eta^2) after any
//! number of bounces inside it (folded into `d` by the material). Chosen against the coating in
//! proportion to the coating's transmittance in the viewing direction.

use super::{BxdfSample, Lobe, LobeFlags, Transport};
use crate::material::fresnel::fresnel_dielectric;
use crate::math::{Color, Vec2, Vec3};
use crate::sampling::warp::cosine_hemisphere;
use std::f32::consts::FRAC_1_PI;

/// f = d (1 - F(wo)) (1 - F(wi)) / pi, with `d` already divided by eta^2 and by the
/// internal-reflection term.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlasticDiffuse {
    pub d: Color,
    pub eta: f32,
    /// Mean of the base's reflectance as given: its sampling weight against the coating's.
    pub d_mean: f32,
}

impl Lobe for PlasticDiffuse {
    #[inline]
    fn lifted(self, wl: &crate::spectrum::Wavelengths, _eta_ratio: f32) -> Self {
        PlasticDiffuse { d: wl.reflectance(self.d), ..self }
    }

    const DIRECTIONAL: bool = true;

    #[inline]
    fn flags(&self) -> LobeFlags {
        LobeFlags::DIFFUSE_REFLECTION
    }

    #[inline]
    fn is_isotropic(&self) -> bool {
        true
    }

    #[inline]
    fn sampling_weight(&self) -> f32 {
        self.d_mean
    }

    #[inline]
    fn selection(&self, wo: Vec3) -> f32 {
        1.0 - fresnel_dielectric(wo.z, self.eta)
    }

    #[inline]
    fn mean_albedo(&self) -> f32 {
        self.d.mean()
    }

    #[inline]
    fn lambert_albedo(&self) -> Option<Color> {
        None
    }

    #[inline]
    fn scaled(self, w: f32) -> Self {
        PlasticDiffuse { d: self.d * Color::splat(w), d_mean: self.d_mean * w, ..self }
    }

    #[inline]
    fn f(&self, wo: Vec3, wi: Vec3, _mode: Transport) -> Color {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Color::ZERO;
        }
        let t = (1.0 - fresnel_dielectric(wo.z, self.eta)) * (1.0 - fresnel_dielectric(wi.z, self.eta));
        self.d * (t * FRAC_1_PI)
    }

    #[inline]
    fn pdf(&self, wo: Vec3, wi: Vec3, _mode: Transport) -> f32 {
        if wi.z > 0.0 && wo.z > 0.0 { wi.z * FRAC_1_PI } else { 0.0 }
    }

    #[inline]
    fn sample(&self, wo: Vec3, _uc: f32, u: Vec2, mode: Transport) -> Option<BxdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = cosine_hemisphere(u);
        let pdf = wi.z * FRAC_1_PI;
        (pdf > 0.0).then(|| BxdfSample {
            wi,
            weight: self.f(wo, wi, mode) / FRAC_1_PI,
            pdf,
            flags: LobeFlags::DIFFUSE_REFLECTION,
        })
    }
}
