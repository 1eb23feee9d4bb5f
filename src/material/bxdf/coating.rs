//! A smooth plastic's coating (Mitsuba 3's `plastic`): mirror reflection weighted by the
//! dielectric Fresnel reflectance. Chosen against the base in proportion to that reflectance in
//! the viewing direction (see `plastic_diffuse`).

use super::{BxdfSample, Lobe, LobeFlags, Transport};
use crate::material::fresnel::{fresnel_dielectric, fresnel_diffuse_reflectance};
use crate::math::{Color, Vec2, Vec3};

/// The coating of relative index `eta`, its reflection scaled by `scale` (Mitsuba's
/// `specular_reflectance`). A delta lobe.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FresnelMirror {
    pub eta: f32,
    pub scale: Color,
}

impl Lobe for FresnelMirror {
    #[inline]
    fn lifted(self, wl: &crate::spectrum::Wavelengths, _eta_ratio: f32) -> Self {
        FresnelMirror { scale: wl.reflectance(self.scale), ..self }
    }

    const DIRECTIONAL: bool = true;

    #[inline]
    fn flags(&self) -> LobeFlags {
        LobeFlags::SPECULAR_REFLECTION
    }

    #[inline]
    fn is_isotropic(&self) -> bool {
        true
    }

    /// Mitsuba's proportion: the coating's mean specular reflectance against the base's mean
    /// reflectance (then times `selection`).
    #[inline]
    fn sampling_weight(&self) -> f32 {
        self.scale.mean()
    }

    #[inline]
    fn selection(&self, wo: Vec3) -> f32 {
        fresnel_dielectric(wo.z, self.eta)
    }

    /// Fresnel reflectance of a coating averaged over directions is about its F_dr.
    #[inline]
    fn mean_albedo(&self) -> f32 {
        self.scale.mean() * fresnel_diffuse_reflectance(self.eta)
    }

    #[inline]
    fn lambert_albedo(&self) -> Option<Color> {
        None
    }

    #[inline]
    fn scaled(self, w: f32) -> Self {
        FresnelMirror { scale: self.scale * Color::splat(w), ..self }
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
        let weight = self.scale * fresnel_dielectric(wo.z, self.eta);
        Some(BxdfSample { wi: Vec3::new(-wo.x, -wo.y, wo.z), weight, pdf: 1.0, flags: LobeFlags::SPECULAR_REFLECTION })
    }
}
