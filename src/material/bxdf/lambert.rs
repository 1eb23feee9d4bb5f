//! Lambertian reflection (the seed report's k_d term, Mitsuba 3's `diffuse`): f = r / pi,
//! sampled by the cosine.

use super::{BxdfSample, Lobe, LobeFlags, Transport, colour_weight};
use crate::math::{Color, Vec2, Vec3};
use crate::sampling::warp::cosine_hemisphere;
use std::f32::consts::FRAC_1_PI;

/// Lambertian reflection with albedo `r`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lambert {
    pub r: Color,
}

impl Lobe for Lambert {
    #[inline]
    fn lifted(self, wl: &crate::spectrum::Wavelengths, _eta_ratio: f32) -> Self {
        Lambert { r: wl.reflectance(self.r) }
    }

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
        colour_weight(self.r)
    }

    #[inline]
    fn mean_albedo(&self) -> f32 {
        self.r.mean()
    }

    #[inline]
    fn lambert_albedo(&self) -> Option<Color> {
        Some(self.r)
    }

    #[inline]
    fn scaled(self, w: f32) -> Self {
        Lambert { r: self.r * Color::splat(w) }
    }

    #[inline]
    fn f(&self, _wo: Vec3, wi: Vec3, _mode: Transport) -> Color {
        if wi.z > 0.0 { self.r * FRAC_1_PI } else { Color::ZERO }
    }

    #[inline]
    fn pdf(&self, _wo: Vec3, wi: Vec3, _mode: Transport) -> f32 {
        if wi.z > 0.0 { wi.z * FRAC_1_PI } else { 0.0 }
    }

    #[inline]
    fn sample(&self, _wo: Vec3, _uc: f32, u: Vec2, _mode: Transport) -> Option<BxdfSample> {
        let wi = cosine_hemisphere(u);
        let pdf = wi.z * FRAC_1_PI;
        (pdf > 0.0).then_some(BxdfSample { wi, weight: self.r, pdf, flags: LobeFlags::DIFFUSE_REFLECTION })
    }
}
