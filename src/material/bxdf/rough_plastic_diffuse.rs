//! A rough plastic's base (Mitsuba 3's `roughplastic`), seen through its rough coating: f =
//! d T(cos wo) T(cos wi) / pi with T the coating's transmittance from its table. Chosen against
//! the coating in proportion to that transmittance in the viewing direction.

use super::{BxdfSample, CoatingTable, Lobe, LobeFlags, Transport};
use crate::math::{Color, Vec2, Vec3};
use crate::sampling::warp::cosine_hemisphere;
use std::f32::consts::FRAC_1_PI;

#[derive(Clone, Copy, Debug)]
pub struct RoughPlasticDiffuse {
    /// The base's reflectance divided by eta^2 and by the internal-reflection term.
    pub d: Color,
    pub table: &'static CoatingTable,
    /// Mean of the base's reflectance as given: its sampling weight against the coating's.
    pub d_mean: f32,
}

impl PartialEq for RoughPlasticDiffuse {
    fn eq(&self, o: &Self) -> bool {
        self.d == o.d && std::ptr::eq(self.table, o.table) && self.d_mean == o.d_mean
    }
}

impl Lobe for RoughPlasticDiffuse {
    #[inline]
    fn lifted(self, wl: &crate::spectrum::Wavelengths, _eta_ratio: f32) -> Self {
        RoughPlasticDiffuse { d: wl.reflectance(self.d), ..self }
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
        self.table.transmittance(wo.z)
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
        RoughPlasticDiffuse { d: self.d * Color::splat(w), d_mean: self.d_mean * w, ..self }
    }

    #[inline]
    fn f(&self, wo: Vec3, wi: Vec3, _mode: Transport) -> Color {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Color::ZERO;
        }
        self.d * (self.table.transmittance(wo.z) * self.table.transmittance(wi.z) * FRAC_1_PI)
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
