//! Perfect mirror reflection with a fixed reflectance (seed eq. 3, the seed report's k_r).

use super::{BxdfSample, Lobe, LobeFlags, Transport, colour_weight, reflect_local};
use crate::math::{Color, Vec2, Vec3};

/// A mirror of reflectance `r`: a delta lobe (f and pdf 0 for any given pair of directions).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mirror {
    pub r: Color,
}

impl Lobe for Mirror {
    #[inline]
    fn lifted(self, wl: &crate::spectrum::Wavelengths, _eta_ratio: f32) -> Self {
        Mirror { r: wl.reflectance(self.r) }
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
        colour_weight(self.r)
    }

    #[inline]
    fn mean_albedo(&self) -> f32 {
        self.r.mean()
    }

    #[inline]
    fn lambert_albedo(&self) -> Option<Color> {
        None
    }

    #[inline]
    fn scaled(self, w: f32) -> Self {
        Mirror { r: self.r * Color::splat(w) }
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
        Some(BxdfSample { wi: reflect_local(wo), weight: self.r, pdf: 1.0, flags: LobeFlags::SPECULAR_REFLECTION })
    }
}
