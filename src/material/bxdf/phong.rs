//! Normalised (energy-conserving) Phong reflection around the mirror direction (Lafortune and
//! Willems 1994): the seed report's highlight term k_s (R . V)^n made a physical lobe,
//! f = ks (n + 2) / (2 pi) cos^n(alpha), alpha the angle between wi and the mirror direction of
//! wo, sampled by cos^n around that direction.

use super::{BxdfSample, Lobe, LobeFlags, Transport, reflect_local};
use crate::math::{Color, Frame, Vec2, Vec3};
use std::f32::consts::PI;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Phong {
    pub ks: f32,
    pub exponent: f32,
}

/// A direction around `r` with density proportional to cos^n of the angle to it.
#[inline]
pub fn sample_phong(r: Vec3, exponent: f32, u: Vec2) -> Vec3 {
    let cos_a = u.x.powf(1.0 / (exponent + 1.0));
    let sin_a = (1.0 - cos_a * cos_a).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Frame::from_z(r).to_world(Vec3::new(sin_a * phi.cos(), sin_a * phi.sin(), cos_a))
}

impl Lobe for Phong {
    #[inline]
    fn lifted(self, _wl: &crate::spectrum::Wavelengths, _eta_ratio: f32) -> Self {
        self
    }

    #[inline]
    fn flags(&self) -> LobeFlags {
        LobeFlags::GLOSSY_REFLECTION
    }

    #[inline]
    fn is_isotropic(&self) -> bool {
        true
    }

    #[inline]
    fn sampling_weight(&self) -> f32 {
        self.ks
    }

    #[inline]
    fn mean_albedo(&self) -> f32 {
        self.ks
    }

    #[inline]
    fn lambert_albedo(&self) -> Option<Color> {
        None
    }

    #[inline]
    fn scaled(self, w: f32) -> Self {
        Phong { ks: self.ks * w, ..self }
    }

    #[inline]
    fn f(&self, wo: Vec3, wi: Vec3, _mode: Transport) -> Color {
        if !(wi.z > 0.0) {
            return Color::ZERO;
        }
        let c = reflect_local(wo).dot(wi);
        if c > 0.0 {
            Color::splat(self.ks * (self.exponent + 2.0) / (2.0 * PI) * c.powf(self.exponent))
        } else {
            Color::ZERO
        }
    }

    #[inline]
    fn pdf(&self, wo: Vec3, wi: Vec3, _mode: Transport) -> f32 {
        if !(wi.z > 0.0) {
            return 0.0;
        }
        let c = reflect_local(wo).dot(wi);
        if c > 0.0 { (self.exponent + 1.0) / (2.0 * PI) * c.powf(self.exponent) } else { 0.0 }
    }

    #[inline]
    fn sample(&self, wo: Vec3, _uc: f32, u: Vec2, mode: Transport) -> Option<BxdfSample> {
        let wi = sample_phong(reflect_local(wo), self.exponent, u);
        let pdf = self.pdf(wo, wi, mode);
        if !(pdf > 0.0) {
            return None;
        }
        let weight = self.f(wo, wi, mode) * (wi.z / pdf);
        Some(BxdfSample { wi, weight, pdf, flags: LobeFlags::GLOSSY_REFLECTION })
    }
}
